"""``automated_calibration`` problem files end to end (Dressler (2012), ch. 5.6, Table 5.7), and their bad input.

Independent references: Table 5.7's calibrated parameters (the truth of the simulated
calibration, from the reference table ``gantry_tau_L1.toml``); the thesis' set-up numbers
(100 desired poses, C = 200); the program files read back by the project's CSV reader.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from gtmodel._tables import read_table
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, SHARED_REFERENCE, assert_bad_problem, assert_bad_problem_through_cli, solve_through_cli
from ...conftest import replace_once as _edit

FILE = PROBLEMS_DIR / "l1_automated_calibration.toml"

#: A cheap variant: a coarser search, 30 desired poses, 2 simulated calibrations.
COARSE = [_edit("search_step = 0.1 ", "search_step = 0.2 "), _edit("desired = 100", "desired = 30"), _edit("runs = 5", "runs = 2")]


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ac")
    text = FILE.read_text()
    for e in COARSE:
        text = e(text)
    f = folder / "coarse.toml"
    f.write_text(text)
    code, summary = solve_through_cli(f, folder / "out", "--no-plots")
    return code, summary, folder / "out"


def test_truth_is_table_5_7_calibrated():
    ref = tomllib.loads((SHARED_REFERENCE / "gantry_tau_L1.toml").read_text())["table_5_7"]
    doc = tomllib.loads(FILE.read_text())
    keys = ("L", "As", "v")
    assert all(np.allclose(doc["truth"][k], ref["calibrated"][k]) and np.allclose(doc["apriori"][k], ref["manual"][k]) for k in keys)
    assert doc["limits"]["joint_angle_max_deg"] == ref["spherical_joint_limit_deg"]
    assert doc["limits"]["safety_margin"] == ref["workspace_safety_distance_m"]


def test_coarse_run_is_accepted_and_writes_the_program(coarse):
    code, s, out = coarse
    assert code == 0 and s["status"] == Status.OPTIMAL, s["message"]
    n = s["n_poses"]
    assert 15 <= n <= 60 and 0 < s["workspace_ratio"] < 1
    table = read_table(out / "poses.csv", what="poses")
    assert table.n_rows == n
    assert (out / "calibration_poses.mod").read_text().count("MoveAbsJ") == n
    arms = [(a["rank"], a["acceptance"] < 200, a["non_identifiable"]) for a in s["arms"]]
    assert arms == [(7, True, [])] * 3, arms
    last = s["rounds"][-1]
    assert last["recovered"] and last["accepted_5_14"]
    cal = s["calibration"]
    assert cal["status"] == "optimal" and cal["source"] == "synthetic" and cal["true_error_mean_m"] < 2 * s["noise_m"]  # 15 poses
    assert (out / "parameters.toml").is_file() and (out / "errors.csv").is_file()


def test_more_poses_when_rejected(tmp_path):
    """A threshold no set can pass: every round asks for growth x more poses, then check_failed."""
    text = FILE.read_text()
    for e in COARSE + [_edit("threshold = 200.0", "threshold = 1.0"), _edit("max_rounds = 4", "max_rounds = 2")]:
        text = e(text)
    f = tmp_path / "strict.toml"
    f.write_text(text)
    code, s = solve_through_cli(f, tmp_path / "out", "--no-plots")
    assert code == 1 and s["status"] == Status.CHECK_FAILED
    assert [r["desired"] for r in s["rounds"]] == [30, 45]
    assert s["rounds"][1]["n_poses"] > s["rounds"][0]["n_poses"]


@pytest.mark.slow
def test_shipped_table_5_7_set_up(tmp_path):
    """About 100 poses, eq. 5.14 passed with C = 200, the simulated calibration recovers the truth."""
    code, s = solve_through_cli(FILE, tmp_path / "out")
    assert code == 0 and s["status"] == Status.OPTIMAL
    assert 80 <= s["n_poses"] <= 130 and s["desired"] == 100
    assert s["max_acceptance"] < 200
    assert s["rounds"][-1]["recovered"]
    assert s["rounds"][-1]["tcp_error_mean_m"] < s["noise_m"]
    assert s["calibration"]["status"] == "optimal" and s["calibration"]["true_error_mean_m"] < s["noise_m"]


@pytest.mark.slow
def test_measured_data_at_the_poses_are_calibrated(tmp_path, coarse):
    """[data]: noise-free measurements of Table 5.7's calibrated robot at the written poses
    give a model that reproduces them (validation error below 1 um)."""
    from gtmodel.calibration.measurements import measurement_columns
    from gtmodel.robots.closure import ThreeLinkClosure
    from gtmodel.robots.parameters import KinematicParameters

    doc = tomllib.loads(FILE.read_text())
    truth = ThreeLinkClosure(KinematicParameters(L=np.array(doc["truth"]["L"]), As=np.array(doc["truth"]["As"]), v=np.array(doc["truth"]["v"])))
    q = read_table(coarse[2] / "poses.csv", what="poses").data[:, 1:4]
    T = np.atleast_2d(truth.fk(q)[0])
    rows = [",".join(measurement_columns())] + [",".join(repr(float(v)) for v in np.r_[a, b]) for a, b in zip(q, T)]
    (tmp_path / "measured.csv").write_text("\n".join(rows) + "\n")
    text = FILE.read_text()
    for e in COARSE:
        text = e(text)
    f = tmp_path / "measured.toml"
    f.write_text(text + '\n[data]\nfile = "measured.csv"\n')
    code, s = solve_through_cli(f, tmp_path / "out", "--no-plots")
    assert code == 0 and s["calibration"]["source"].endswith("measured.csv")
    assert s["calibration"]["validation_error_max_m"] < 1e-6


BAD = [
    ("obstacle_swallows", _edit('name = "table"\nlo = [1.9, -1.6, -0.6]\nhi = [3.0, -0.6, 0.35]', 'name = "table"\nlo = [-5, -5, -5]\nhi = [5, 5, 5]'),
     r"field 'obstacles\[0\]': expected an obstacle that leaves part of the workspace"),
    ("camera_sees_nothing", _edit("look_at = [1.5, -0.7, 0.55]", "look_at = [1.5, 10.0, 0.55]"), r"field 'device': expected a device that measures"),
    ("camera_without_look_at", _edit("look_at = [1.5, -0.7, 0.55]\n", ""), r"field 'device\.look_at'"),
    ("obstacle_inverted", _edit("hi = [3.0, -0.6, 0.35]", "hi = [1.0, -0.6, 0.35]"), r"field 'obstacles\[0\]\.hi'"),
    ("travel_reversed", _edit("cart_travel = [[-1.0, 1.0], [-1.0, 1.0]", "cart_travel = [[1.0, -1.0], [-1.0, 1.0]"), r"field 'limits\.cart_travel\[0\]'"),
    ("nan_apriori", _edit("L  = [2.05, 1.82, 1.81]", "L  = [2.05, nan, 1.81]"), r"field 'apriori\.L'"),
    ("zero_length", _edit("L  = [2.05, 1.82, 1.81]", "L  = [2.05, 0.0, 1.81]"), r"field 'apriori\.L': expected 3 positive"),
    ("bad_direction", _edit("v  = [[1.0, 0.0, 0.0], [1.0", "v  = [[0.1, 0.0, 0.0], [1.0"), r"field 'apriori\.v': expected guideway directions"),
    ("no_limits_left", _edit("joint_angle_max_deg = 30.0", "joint_angle_max_deg = 0.5"), r"field 'limits': expected limits that leave"),
    ("nan_noise", _edit('type = "camera"', 'type = "camera"\nnoise = nan'), r"field 'device\.noise'"),
    ("zero_desired", _edit("desired = 100", "desired = 0"), r"field 'poses\.desired'"),
    ("growth_one", _edit("growth = 1.5", "growth = 1.0"), r"field 'poses\.growth'"),
    ("tracker_range_reversed", _edit('type = "camera"', 'type = "laser_tracker"\nrange = [10.0, 1.0]'), r"field 'device\.range'"),
    ("tracker_out_of_range", _edit('type = "camera"', 'type = "laser_tracker"\nrange = [30.0, 40.0]'), r"field 'device': expected a device that measures"),
    ("missing_data_file", lambda t: t + '\n[data]\nfile = "no_such.csv"\n', r"field 'data\.file'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_input_names_the_field(tmp_path, case, edit, match):
    assert_bad_problem(tmp_path, FILE, case, edit, match)


def test_swallowing_obstacle_exits_2_through_the_cli(tmp_path, capsys):
    _, edit, match = BAD[0]
    assert_bad_problem_through_cli(tmp_path, capsys, edit(FILE.read_text()), match)
