"""Kind ``correction_stability``: the shipped problem end to end, its tables, the thesis structure, bad input.

Independent references: the Table 14 CSV re-read against summary.json (a second reading of
the run), the pole cross-check against the simulated gains (a second method), the rigid
delay-integrator limit ``2 sin(pi/50)`` bounding every gain (closed form), and Cvitanic
(2021), Table 14's structure (x gains >= 5x y gains), held as a strict xfail: the
physically documented model of this package does not produce it (see the test's reason).
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from gtmodel.problems import run_problem

from ...conftest import PROBLEMS_DIR, assert_bad_problem_through_cli, replace_once as _edit

FILE = PROBLEMS_DIR / "kr500_correction_stability.toml"
RIGID_CRITICAL_GAIN = 2 * math.sin(math.pi / 50)  # K z/(z-1) z^-13 around a plant of gain 1


@pytest.fixture(scope="module")
def shipped(tmp_path_factory):
    out = tmp_path_factory.mktemp("correction")
    return run_problem(FILE, out, plots=True), out


@pytest.mark.slow  # the shipped run: ~10 CPU-s
def test_shipped_problem_runs(shipped):
    outcome, out = shipped
    assert outcome.exit_code == 0 and outcome.summary["status"] == "completed"
    files = ["summary.json", "calibration_fits.csv", "gains.png", "loop_error.png", "offset_response.png", "table_14.csv", "table_14.md"]
    assert sorted(outcome.summary["files"]) == sorted(files)
    assert all((out / f).stat().st_size > 0 for f in files)


@pytest.mark.slow  # the shipped run: ~10 CPU-s
def test_summary_has_the_gains_per_validation_pose(shipped):
    s = json.loads((shipped[1] / "summary.json").read_text())
    assert len(s["validation"]) == 6
    keys = [(sorted(p["predicted_gain"]), sorted(p["simulated_gain"])) for p in s["validation"]]
    assert keys == [(["x", "y"], ["x", "y"])] * 6
    assert s["predicted_gain"]["y"] == [p["predicted_gain"]["y"] for p in s["validation"]]
    assert len(s["calibration_fits"]) == 16 and len(s["assumptions"]) >= 5


@pytest.mark.slow  # the shipped run: ~10 CPU-s
def test_table_14_csv_is_the_summary(shipped):
    # second reading: the CSV's gains are summary.json's
    _, out = shipped
    s = json.loads((out / "summary.json").read_text())
    with open(out / "table_14.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 6
    np.testing.assert_allclose([float(r["predicted_y"]) for r in rows], s["predicted_gain"]["y"], rtol=1e-3)
    np.testing.assert_allclose([float(r["simulated_x"]) for r in rows], s["simulated_gain"]["x"], rtol=1e-3)
    assert sum(r["within_one_increment"] == "yes" for r in rows) == s["poses_within_one_increment"]


@pytest.mark.slow  # the shipped run: ~10 CPU-s
def test_poles_confirm_the_simulated_gains(shipped):
    # second method: the closed-loop poles give the same grid gains as the step-by-step simulation
    s = shipped[0].summary
    assert s["methods_agree"]
    crit = np.array([[p[key][d] for d in ("x", "y")] for p in s["validation"] for key in ("predicted_critical_gain", "simulated_critical_gain")])
    assert np.all(crit < RIGID_CRITICAL_GAIN)  # closed form: the structure only lowers the rigid limit


@pytest.mark.slow  # the shipped run: ~10 CPU-s
def test_prediction_within_one_increment_at_5_of_6_poses(shipped):
    # Table 14's second claim (judged): the single-mode GPR prediction against the richer simulation
    assert shipped[0].summary["poses_within_one_increment"] >= 5


@pytest.mark.slow  # the shipped run: ~10 CPU-s
@pytest.mark.xfail(strict=True, reason=(
    "Table 14's x gains >= 5x y gains do not come out of the documented model: a pose-offset command is executed "
    "(DC gain 1 in every direction) and the 52 ms delay puts the phase crossover (~5 Hz) below the structural modes "
    "(dominant 12-26 Hz, second 36-78 Hz), so both directions sit near the delay-integrator limit 2 sin(pi/50) = 0.126; measured x/y = 0.83-0.91. "
    "The thesis' ratio must come from measured x responses we do not have; not tuned in."))
def test_x_gains_at_least_5x_y_gains(shipped):
    s = shipped[0].summary
    ratio = np.array(s["x_over_y_predicted"])
    assert np.all(ratio >= 5.0), ratio


BAD = [
    ("pose_outside_joint_limits", _edit("[-33.96, 113.53]", "[-150.0, 113.53]"),
     r"field 'poses\.calibration_deg\[0\]': pose: row 0: joint 2 = -150 deg is outside the joint limits -130\.\.20 deg"),
    ("validation_outside_joint_limits", _edit("[-51.27, 89.57]", "[-51.27, 150.0]"),
     r"field 'poses\.validation_deg\[5\]': .*joint 3 = 150 deg is outside the joint limits -100\.\.144 deg"),
    ("wrist_outside_joint_limits", _edit("[0.0, 0.0, -60.0, 0.0]", "[0.0, 0.0, -125.0, 0.0]"),
     r"field 'poses\.calibration_deg\[0\]': .*joint 5 = -125 deg is outside"),
    ("negative_offset", _edit("offset = 1.0e-4", "offset = -1.0e-4"), r"field 'calibration\.offset': expected a positive number, got -0\.0001"),
    ("negative_resolution", _edit("resolution_y = 0.01", "resolution_y = -0.01"), r"field 'loop\.resolution_y': expected a positive number"),
    ("negative_feed", _edit("feed_rate = 0.04233", "feed_rate = -0.04233"), r"field 'path\.feed_rate': expected a positive number"),
    ("short_duration", _edit("duration = 10.0", "duration = 3.0"), r"field 'loop\.duration': expected at least two path periods \(4\.82"),
    ("too_fine_grid", _edit("resolution_y = 0.01", "resolution_y = 1e-6"), r"field 'loop\.resolution_y': expected a step giving at most 10000"),
    ("unknown_direction", _edit('directions = ["x", "y"]', 'directions = ["x", "w"]'), r"field 'loop\.directions\[1\]': expected one of x, y, z"),
    ("repeated_direction", _edit('directions = ["x", "y"]', 'directions = ["y", "y"]'), r"field 'loop\.directions': expected distinct directions"),
    ("two_calibration_poses", lambda t: t.replace(t[t.index("calibration_deg = ["):t.index("# Table 13")],
                                                  "calibration_deg = [[-33.96, 113.53], [-31.26, 98.33]]\n"),
     r"field 'poses\.calibration_deg': expected at least 3 distinct"),
    ("zero_delay", _edit("delay_cycles = 13", "delay_cycles = 0"), r"field 'loop\.delay_cycles': expected an integer in 1\.\.250"),
    ("unknown_arm", _edit('model = "serial_6r_illustrative"', 'model = "kr1000"'), r"field 'arm\.model': expected a shipped set"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[b[0] for b in BAD])
def test_bad_input_through_the_cli(tmp_path, capsys, case, edit, match):
    """Each bad input: exit 2, one message naming the file and the field."""
    assert_bad_problem_through_cli(tmp_path, capsys, edit(FILE.read_text()), match)
