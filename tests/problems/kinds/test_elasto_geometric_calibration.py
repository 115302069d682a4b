"""Kind ``elasto_geometric_calibration``: the shipped problem end to end, and bad input.

Independent references: the synthetic truth's own validation error on the same noisy poses
(the noise floor, as the L1 kinematic calibration test), the true compliances that
generated the data, and the D1's measured TCP stiffness (2-4 N/um, reference table).
"""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from gtmodel.calibration.measurements import read_measurements
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem, run_problem
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, replace_once as _edit

FILE = PROBLEMS_DIR / "l1_elasto_geometric.toml"
#: Elasto-geometric validation mean error vs the noise floor (true model on the same poses).
NOISE_FLOOR_RTOL = 0.05
#: Geometric-only vs elasto-geometric mean error on the two-load data: at least this ratio.
IMPROVEMENT_RATIO = 3.0
#: Calibrated compliances within this many standard deviations of the truth.
N_SIGMA = 3.0
#: Load step between the payloads vs m g with g = 9.81 m/s^2 (the parameter set's g).
PAYLOAD_WEIGHT_RTOL = 1e-9
#: Longest accepted time to reject a bad file [s].
REJECT_SECONDS = 5.0


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("l1eg")
    outcome = run_problem(FILE, out)
    return outcome.exit_code, out, outcome.summary


def test_shipped_problem_is_optimal_with_the_required_summary(solved):
    code, out, s = solved
    assert code == 0
    assert s["status"] == "optimal"


@pytest.mark.parametrize(
    "key",
    ["geometric_mean_error_m", "geometric_max_error_m", "elasto_geometric_mean_error_m",
     "elasto_geometric_max_error_m", "noise_floor_mean_error_m", "noise_floor_max_error_m",
     "improvement_mean_error_m", "identifiability", "load_identifiability", "compliances",
     "stiffness_values", "stiffness_map", "single_load", "payloads_kg"],
)
def test_shipped_problem_summary_has_the_required_key(solved, key):
    _, _, s = solved
    assert key in s, key


@pytest.mark.parametrize(
    "name",
    ["parameters.toml", "errors.csv", "error_histogram.png", "stiffness_map.png",
     "calibration_measurements.csv", "validation_measurements.csv"],
)
def test_shipped_problem_writes_the_result_file(solved, name):
    _, out, _ = solved
    assert (out / name).stat().st_size > 0


def test_stopped_calibration_writes_no_parameter_set(tmp_path):
    """max_iter = 1 stops the LM early: status max_iterations, exit 1, and no
    parameters.toml (a last iterate is not handed on as a calibrated robot)."""
    f = tmp_path / "stopped.toml"
    f.write_text(_edit("max_iter = 200", "max_iter = 1")(FILE.read_text()))
    outcome = run_problem(f, tmp_path / "out", plots=False)
    code, s = outcome.exit_code, outcome.summary
    assert code == 1
    assert s["status"] == "max_iterations"
    assert not (tmp_path / "out" / "parameters.toml").exists()
    assert "parameters.toml" not in s["files"]


def test_elasto_geometric_reaches_the_noise_floor_and_beats_the_geometric_model(solved):
    _, _, s = solved
    floor = s["noise_floor_mean_error_m"]
    assert abs(s["elasto_geometric_mean_error_m"] - floor) <= NOISE_FLOOR_RTOL * floor
    assert s["geometric_mean_error_m"] >= IMPROVEMENT_RATIO * s["elasto_geometric_mean_error_m"]
    assert s["mean_error_m"] == s["elasto_geometric_mean_error_m"]


def test_written_measurements_carry_the_plate_load(solved):
    """The calibration/validation CSV files read back with the load columns: two plate loads
    (without and with the declared payload), their difference the payload's weight (m g)."""
    _, out, s = solved
    cal = read_measurements(out / "calibration_measurements.csv")
    val = read_measurements(out / "validation_measurements.csv")
    assert cal.n_poses == s["n_calibration"] and val.n_poses == s["n_validation"]
    assert cal.has_load and val.has_load and cal.n_q == 3
    Fz = np.unique(cal.load[:, 2])
    assert Fz.size == 2
    assert Fz[1] - Fz[0] == pytest.approx(9.81 * max(s["payloads_kg"]), rel=PAYLOAD_WEIGHT_RTOL)


def test_compliances_identifiable_with_the_geometry(solved):
    _, _, s = solved
    ident = s["identifiability"]
    assert ident["rank"] == ident["n_parameters"] == 27 and ident["non_identifiable"] == []
    assert all(abs(row["z"]) < N_SIGMA for row in s["compliances"])
    single = s["single_load"]["load_identifiability"]
    assert single["rank"] == single["n_parameters"] - 1 and single["explanations"]


def test_stiffness_map_is_reported_with_the_measured_figure(solved):
    _, _, s = solved
    m = s["stiffness_map"]
    assert m["measured_D1_N_per_um"] == [2.0, 4.0]
    assert 0 < m["min_eigenvalue_N_per_um"][0] <= m["axis_N_per_um"]["z"][0]
    assert s["stiffness_values"]["k_joint_N_per_m"] == 1.15e8


BAD = [
    ("negative_payload", _edit("payloads_kg = [0.0, 40.0]", "payloads_kg = [0.0, -40.0]"), r"field 'truth\.payloads_kg'"),
    ("unknown_field", _edit("seed = 0", "seed = 0\nsead = 1"), r"unknown field 'truth\.sead'"),
    ("bad_stiffness_file", _edit('stiffness = "stiffness"', 'stiffness = "nothing.toml"'), r"field 'truth\.stiffness'"),
    ("bad_pattern", _edit('free_compliance = ["c_l*", "c_a*"]', 'free_compliance = ["k*"]'), r"field 'calibration\.free_compliance'"),
    ("bad_noise", _edit('noise = "laser_tracker"', 'noise = "ruler"'), r"field 'truth\.noise'"),
    ("bad_start_compliance", _edit('compliance = "zero"', 'compliance = "half"'), r"field 'start\.compliance'"),
    ("coarse_grid", _edit("grid_step = 0.1153", "grid_step = 0.9"), r"field 'truth\.grid_step'"),
    ("bad_parameter_set", _edit('parameters = "L1"', 'parameters = "L9"'), r"field 'truth\.parameters'"),
    ("negative_map_step", _edit("step = 0.05", "step = -0.05"), r"field 'stiffness_map\.step'"),
    ("payloads_string", _edit("payloads_kg = [0.0, 40.0]", 'payloads_kg = "heavy"'), r"field 'truth\.payloads_kg'"),
    ("payloads_huge", _edit("payloads_kg = [0.0, 40.0]", "payloads_kg = [0.0, 1e308]"), r"field 'truth\.payloads_kg'"),
    ("payloads_empty", _edit("payloads_kg = [0.0, 40.0]", "payloads_kg = []"), r"field 'truth\.payloads_kg'"),
    ("grid_step_tiny", _edit("grid_step = 0.1153", "grid_step = 1e-7"), r"field 'truth\.grid_step': expected a grid step giving at most"),
    ("grid_step_fine", _edit("grid_step = 0.1153", "grid_step = 0.005"), r"field 'truth\.grid_step': expected a grid step giving at most"),
    ("grid_step_nan", _edit("grid_step = 0.1153", "grid_step = nan"), r"field 'truth\.grid_step': expected a finite number"),
    ("map_step_tiny", _edit("step = 0.05", "step = 1e-6"), r"field 'stiffness_map\.step': expected a step giving at most"),
    ("map_x_outside", _edit("step = 0.05", "step = 0.05\nx = 100.0"), r"field 'stiffness_map\.x'"),
    ("free_compliance_number", _edit('free_compliance = ["c_l*", "c_a*"]', "free_compliance = 1.0"), r"field 'calibration\.free_compliance': expected a list of strings"),
    ("free_compliance_nested", _edit('free_compliance = ["c_l*", "c_a*"]', 'free_compliance = [["c_l*"]]'), r"field 'calibration\.free_compliance"),
    ("seed_bool", _edit("seed = 0", "seed = true"), r"field 'truth\.seed': expected an integer"),
    ("max_iter_huge", _edit("max_iter = 200", "max_iter = 1e308"), r"field 'calibration\.max_iter'"),
    ("single_load_string", _edit("compare_single_load = true", 'compare_single_load = "yes"'), r"field 'calibration\.compare_single_load'"),
]


@pytest.mark.parametrize("case, edit, match", BAD, ids=[c[0] for c in BAD])
def test_bad_files(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(FILE.read_text()))
    t0 = time.perf_counter()
    with pytest.raises(ProblemError, match=match) as info:
        load_problem(f)
    assert time.perf_counter() - t0 < REJECT_SECONDS
    assert str(f) in str(info.value).splitlines()[0]


def test_bad_file_gives_invalid_input(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(FILE.read_text().replace("payloads_kg = [0.0, 40.0]", 'payloads_kg = "heavy"'))
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.status == Status.INVALID_INPUT and outcome.exit_code == 2
    assert re.search(r"payloads_kg", outcome.summary["message"])
    assert outcome.summary["files"] == ["summary.json"]


def test_grid_step_1e_300_is_bounded_up_front(tmp_path):
    f = tmp_path / "tiny.toml"
    f.write_text(_edit("grid_step = 0.1153", "grid_step = 1e-300")(FILE.read_text()))
    with pytest.raises(ProblemError, match=r"field 'truth\.grid_step': expected a grid step giving at most"):
        load_problem(f)
