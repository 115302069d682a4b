"""Kind ``replay`` (formerly ``tracking``): the shipped replay end to end, a replayed trajectory file, bad input.

Independent references: the summary figures recomputed from ``tracking.csv`` (a second
reading of the run), the static actuator error after the settling hold against the closed
form ``(b/(1-a) - 1) Delta q`` of (6.11), and the reference columns against the trajectory
``l1_time_optimal`` writes on its own.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, run_problem
from gtmodel.problems.kinds.replay import ReplayDeclaration
from gtmodel.robots import GantryTau3Kinematics
from gtmodel.status import Status

from gtmodel.cli import EXIT_BAD_INPUT

from ...conftest import PROBLEMS_DIR, REPO, assert_bad_problem, replace_once as _edit, solve_through_cli

TRACKING_FILE = PROBLEMS_DIR / "l1_tracking.toml"
DC_GAINS = np.array([0.03527 / (1 - 0.9647), 0.03425 / (1 - 0.9656), 0.02748 / (1 - 0.9728)])
#: Residual lag after 1 s of hold: the slowest pole 0.9728^250 = 1e-3 of a lag of up to 0.1 m.
SETTLE_RESIDUAL_M = 2e-4
T_START = np.array([0.0, 2.9, -0.5])


@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    out = tmp_path_factory.mktemp("tracking")
    outcome = run_problem(TRACKING_FILE, out, plots=True)
    return outcome, out


def test_shipped_tracking_problem_runs(shipped):
    outcome, out = shipped
    assert outcome.exit_code == 0 and outcome.summary["status"] == "completed"
    assert outcome.summary["files"] == ["summary.json", "actuator_error.png", "deflection.png", "tool_error.png", "tool_path.png", "tracking.csv"]
    assert all((out / f).stat().st_size > 0 for f in outcome.summary["files"])
    s = json.loads((out / "summary.json").read_text())
    assert s["source_status"] == "optimal" and s["samples"] == s["motion_samples"] + 250
    np.testing.assert_allclose(s["structure_modes_hz"], [7.4, 11.5], rtol=1e-12)


def test_summary_figures_are_those_of_tracking_csv(shipped):
    # second reading: max and RMS recomputed from the written table
    outcome, out = shipped
    s = outcome.summary
    with open(out / "tracking.csv") as fh:
        header = fh.readline().strip().split(",")
    data = np.loadtxt(out / "tracking.csv", delimiter=",", skiprows=1)
    col = {h: data[:, k] for k, h in enumerate(header)}
    e_q = np.column_stack([col[f"q{i}"] - col[f"q_ref{i}"] for i in (1, 2, 3)])
    e_T = np.column_stack([col[c] - col[f"{c}_ref"] for c in "xyz"])
    np.testing.assert_allclose(s["actuator_error_max_m"], np.abs(e_q).max(axis=0), rtol=1e-8)
    np.testing.assert_allclose(s["actuator_error_rms_m"], np.sqrt((e_q**2).mean(axis=0)), rtol=1e-8)
    np.testing.assert_allclose(s["tool_error_max_m"], np.abs(e_T).max(axis=0), rtol=1e-6)
    np.testing.assert_allclose(s["tool_error_rms_m"], np.sqrt((e_T**2).mean(axis=0)), rtol=1e-6)
    assert s["deflection_max_m"][0] < s["deflection_max_m"][1]  # stiffer in x


def test_final_actuator_error_is_the_dc_gain_error(shipped):
    # closed form of (6.11): a held reference settles at b/(1-a) times the move
    r = shipped[0].solution.response
    move = r.q_ref[-1] - r.q_ref[0]
    np.testing.assert_allclose(r.actuator_error[-1], (DC_GAINS - 1) * move, atol=SETTLE_RESIDUAL_M)


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_replayed_reference_is_the_time_optimal_trajectory(shipped, tmp_path):
    # independent: the trajectory l1_time_optimal writes when solved on its own
    outcome, _ = shipped
    ref = run_problem(PROBLEMS_DIR / "l1_time_optimal.toml", tmp_path / "p2p", plots=False)
    data = np.loadtxt(tmp_path / "p2p" / "trajectory.csv", delimiter=",", skiprows=1)
    r = outcome.solution.response
    n = data.shape[0]
    assert ref.exit_code == 0 and outcome.solution.motion_samples == n
    np.testing.assert_allclose(r.q_ref[:n], data[:, 4:7], atol=1e-9)
    np.testing.assert_allclose(r.T_ref[:n], data[:, 1:4], atol=1e-6)


def _trajectory(path, dt=0.004, n=150, drop=None, shift=0.0, last=None):
    """A smooth 10 mm motion in x from T_START as a trajectory.csv (columns t, x, y, z, q1..q3)."""
    kin = GantryTau3Kinematics("L1")
    t = np.arange(n) * dt
    if last is not None:
        t[-1] = t[-2] + last
    s = np.clip(t / t[-1], 0, 1)
    T = T_START + np.outer(0.01 * (10 * s**3 - 15 * s**4 + 6 * s**5), [1.0, 0.0, 0.0])
    q = kin.ik(T)
    cols = {"t": t, "x": T[:, 0] + shift, "y": T[:, 1], "z": T[:, 2], "q1": q[:, 0], "q2": q[:, 1], "q3": q[:, 2]}
    if drop:
        cols.pop(drop)
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="", fmt="%.12g")
    return path


def _file_problem(csv) -> str:
    return _edit('problem = "l1_time_optimal.toml"', f'file = "{csv}"')(TRACKING_FILE.read_text())


def test_trajectory_file_is_replayed(tmp_path):
    csv = _trajectory(tmp_path / "traj.csv", last=0.0013)  # last step shorter: a final time, accepted
    f = tmp_path / "file.toml"
    f.write_text(_file_problem(csv))
    d = load_problem(f).declaration
    assert isinstance(d, ReplayDeclaration) and d.source == csv
    code, summary = solve_through_cli(f, tmp_path / "out", "--no-plots")
    assert code == 0 and summary["status"] == "completed" and summary["source_status"] == "file"
    assert summary["motion_samples"] == 150 and summary["accelerometer_clipped_samples"] == 0
    # a 10 mm move: the static actuator errors are (b/(1-a) - 1) of the cart moves, below 0.2 mm
    assert max(abs(e) for e in summary["actuator_error_final_m"]) < 2e-4


def test_wrong_sample_time_through_the_cli(tmp_path):
    # the command itself: `python -m gtmodel.cli solve`, exit 2, one message naming both files and the field
    csv = _trajectory(tmp_path / "traj5ms.csv", dt=0.005)
    f = tmp_path / "bad.toml"
    f.write_text(_file_problem(csv))
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    proc = subprocess.run([sys.executable, "-m", "gtmodel.cli", "solve", str(f), "--out", str(tmp_path / "out"), "--quiet"],
                          capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == EXIT_BAD_INPUT == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = [line for line in proc.stderr.splitlines() if "trajectory.file" in line]
    assert len(lines) == 1, proc.stderr
    assert re.search(rf"{f}: field 'trajectory\.file': expected samples dt = 0\.004 s apart, column t \(the trajectory file {csv}: step 0\.005 s", lines[0]), lines[0]
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["status"] == "invalid_input"


CSV_BAD = [
    ("missing_column", {"drop": "q2"}, r"field 'trajectory\.file': expected the columns t, x, y, z, q1, q2, q3 \(.*traj\.csv lacks q2\)"),
    ("missing_t", {"drop": "t"}, r"field 'trajectory\.file': expected the columns .* lacks t\)"),
    ("sample_time", {"dt": 0.002}, r"field 'trajectory\.file': expected samples dt = 0\.004 s apart"),
    ("last_step_longer", {"last": 0.006}, r"field 'trajectory\.file': expected samples dt = 0\.004 s apart.*step 0\.006 s after row 149"),
    ("one_row", {"n": 1}, r"field 'trajectory\.file': expected 2 to 900000 samples"),
    ("another_robot", {"shift": 1e-3}, r"field 'trajectory\.file': expected x, y, z = fk\(q1, q2, q3\) of robot\.parameters within 1e-06 m"),
]


@pytest.mark.parametrize("case, kwargs, match", CSV_BAD, ids=[c[0] for c in CSV_BAD])
def test_bad_trajectory_file(tmp_path, case, kwargs, match):
    if kwargs.get("n") == 1:
        (tmp_path / "traj.csv").write_text("t,x,y,z,q1,q2,q3\n0,0,2.9,-0.5,0,0,0\n")
        csv = tmp_path / "traj.csv"
    else:
        csv = _trajectory(tmp_path / "traj.csv", **kwargs)
    base = tmp_path / "base.toml"
    base.write_text(_file_problem(csv))
    assert_bad_problem(tmp_path, base, case, lambda text: text, match)


def test_non_finite_value_in_the_trajectory_file(tmp_path):
    csv = tmp_path / "traj.csv"
    csv.write_text("t,x,y,z,q1,q2,q3\n0,0,2.9,-0.5,0,0,0\n0.004,nan,2.9,-0.5,0,0,0\n")
    base = tmp_path / "base.toml"
    base.write_text(_file_problem(csv))
    assert_bad_problem(tmp_path, base, "nan", lambda text: text, r"field 'trajectory\.file': expected a readable CSV table \(.*traj\.csv: line 3, column 'x': NaN/inf is not allowed")


BAD = [
    ("both_sources", _edit('problem = "l1_time_optimal.toml"', 'problem = "l1_time_optimal.toml"\nfile = "x.csv"'), r"field 'trajectory': expected exactly one of trajectory\.problem"),
    ("no_source", _edit('problem = "l1_time_optimal.toml"', ""), r"field 'trajectory': expected exactly one of trajectory\.problem"),
    ("missing_problem", _edit('problem = "l1_time_optimal.toml"', 'problem = "nowhere.toml"'), r"field 'trajectory\.problem': expected an existing file"),
    ("missing_file", _edit('problem = "l1_time_optimal.toml"', 'file = "nowhere.csv"'), r"field 'trajectory\.file': expected an existing file"),
    ("wrong_kind", _edit('problem = "l1_time_optimal.toml"', 'problem = "l1_calibration.toml"'), r"field 'trajectory\.problem': expected a problem file of kind point_to_point or path_constrained \(.*l1_calibration\.toml is of kind 'calibration'\)"),
    ("kind_is_a_list", lambda text: text.replace('problem = "l1_time_optimal.toml"', 'problem = "listkind.toml"'),
     r"field 'trajectory\.problem': expected a problem file of kind .*listkind\.toml is of kind a list, not a kind name\)"),
    ("itself", _edit('problem = "l1_time_optimal.toml"', 'problem = "l1_tracking.toml"'), r"field 'trajectory\.problem': expected a problem file of kind point_to_point or path_constrained"),
    ("unknown_field", _edit("settle_time = 1.0", "settle_time = 1.0\nsettle = 2.0"), r"unknown field 'trajectory\.settle' \(allowed here: file, problem, settle_time\)"),
    ("unknown_table", _edit("[sensors]", "[sensor]"), r"unknown field 'sensor'"),
    ("settle_negative", _edit("settle_time = 1.0", "settle_time = -1.0"), r"field 'trajectory\.settle_time': expected a non-negative number"),
    ("settle_huge", _edit("settle_time = 1.0", "settle_time = 1e308"), r"field 'trajectory\.settle_time': expected a number <= 60"),
    ("damping_one", _edit("damping = [0.05, 0.05]", "damping = [1.0, 0.05]"), r"field 'structure\.damping': expected numbers of magnitude <= 0\.999"),
    ("frequency_negative", _edit("frequencies_hz = [7.4, 11.5]", "frequencies_hz = [-7.4, 11.5]"), r"field 'structure\.frequencies_hz': expected 2 positive numbers"),
    ("stiffness_short", _edit("stiffness = [4.0e6, 2.0e6]", "stiffness = [4.0e6]"), r"field 'structure\.stiffness': expected a list of 2 finite numbers"),
    ("mass_zero", _edit("mass = 22.38", "mass = 0.0"), r"field 'structure\.mass': expected a positive number"),
    ("noise_negative", _edit("accelerometer_noise = 0.07", "accelerometer_noise = -0.07"), r"field 'sensors\.accelerometer_noise': expected a non-negative number"),
    ("range_zero", _edit("accelerometer_range = 14.709975", "accelerometer_range = 0.0"), r"field 'sensors\.accelerometer_range': expected a positive number"),
    ("seed_bool", _edit("seed = 0", "seed = true"), r"field 'sensors\.seed': expected an integer in 0\.\."),
    ("bad_dynamics", _edit('dynamics_models = "L1_dynamics_models"', 'dynamics_models = "L9_models"'), r"field 'robot\.dynamics_models': expected a shipped set \(L1_dynamics_models\) or an existing file"),
    ("bad_robot", _edit('parameters = "L1"', 'parameters = "Z9"'), r"field 'robot\.parameters'"),
    ("configuration_out_of_range", _edit("configuration = 0", "configuration = 8"), r"field 'robot\.configuration': expected an integer in 0\.\.7"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_tracking_problem(tmp_path, case, edit, match):
    for name in ("l1_time_optimal.toml", "l1_calibration.toml", "l1_tracking.toml"):  # copies: a data file stays in the problem's folder
        (tmp_path / name).write_text((PROBLEMS_DIR / name).read_text())
    (tmp_path / "listkind.toml").write_text((PROBLEMS_DIR / "l1_time_optimal.toml").read_text().replace('kind = "point_to_point"', 'kind = ["point_to_point"]'))
    assert_bad_problem(tmp_path, TRACKING_FILE, case, edit, match)


def test_invalid_referenced_problem_is_named_with_its_field(tmp_path):
    bad = tmp_path / "l1_time_optimal.toml"
    bad.write_text(_edit("end   = [ 0.20, 3.00, -0.60]", "end = [0.2, 9.0, -0.6]")((PROBLEMS_DIR / "l1_time_optimal.toml").read_text()))
    with pytest.raises(ProblemError, match=r"field 'trajectory\.problem': .*l1_time_optimal\.toml: field 'motion\.end'") as info:
        f = tmp_path / "t.toml"
        f.write_text(TRACKING_FILE.read_text())
        load_problem(f)
    assert str(tmp_path / "t.toml") in str(info.value)


def test_status_is_an_enum_member(shipped):
    assert shipped[0].status is Status.COMPLETED


def test_former_kind_name_is_read_as_replay_with_a_deprecation_warning(tmp_path, caplog):
    # the L1 replay was kind "tracking" (issue 45): such a file still loads, as the replay, and says so in the log
    for name in ("l1_time_optimal.toml", "l1_calibration.toml"):
        (tmp_path / name).write_text((PROBLEMS_DIR / name).read_text())
    old = tmp_path / "old.toml"
    old.write_text(TRACKING_FILE.read_text().replace('kind = "replay"', 'kind = "tracking"'))
    with caplog.at_level("WARNING", logger="gtmodel"):
        problem = load_problem(old)
    assert problem.kind == "replay" and isinstance(problem.declaration, ReplayDeclaration)
    assert any("kind = 'tracking' is deprecated: it is now kind = 'replay'" in r.getMessage() and str(old) in r.getMessage()
               for r in caplog.records)
