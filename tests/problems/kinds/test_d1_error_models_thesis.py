"""``problems/thesis/d1_error_models_thesis.toml``: the D1 error models with the thesis' set-up (slow: ~30 s).

Independent references: Dressler (2012), section 5.3 (61 calibration poses of a grid inside the
surveyed cart range, half for validation), Fig. 4.7 (the measured plate orientation varies by
0.1-0.5 deg), Table 5.8 (the final cost per arm is the sum of squared closure residuals, so its
RMS is ``sqrt(V / N)``), and the generating model (ActuatorErrors.table_4_1 with the declared
period, recomputed here for the data).
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from gtmodel.calibration import ActuatorErrors, synthetic_measurements
from gtmodel.problems import load_problem, run_problem
from gtmodel.report.fidelity_d1 import d1_rows, extract
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR

pytestmark = pytest.mark.slow
FILE = PROBLEMS_DIR / "thesis" / "d1_error_models_thesis.toml"


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("d1_thesis")
    outcome = run_problem(FILE, out, plots=False)
    return outcome.status, {m["name"].split(":")[0]: m for m in outcome.summary["models"]}, outcome.summary, out


def test_thesis_pose_count_and_status(solved):
    status, _, s, _ = solved
    assert status == Status.OPTIMAL
    assert (s["n_calibration"], s["n_validation"]) == (63, 63)  # thesis: 61 calibrate, half validate


def test_plate_orientation_varies_as_fig_4_7(solved):
    rng = solved[2]["measured_orientation_range_deg"]
    assert 0.25 <= max(rng) <= 1.0 and min(rng) >= 0.1  # Fig. 4.7: 0.1 (alpha) to 0.5 (beta) deg


def test_link_residual_is_the_rms_of_the_arm_cost(solved):
    # 3-link model: one link per arm, so RMS = sqrt(V_arm / N) (Table 5.8's final cost)
    m1, n = solved[1]["1"], solved[2]["n_calibration"]
    assert np.asarray(m1["link_residual_rms_m2"]) == pytest.approx(np.sqrt(np.asarray(m1["cost_per_arm"]) / n), rel=1e-9)


def test_plate_joints_are_what_the_six_link_data_barely_determine(solved):
    models = solved[1]
    free, held = models["3"], models["3, plate joints B0 held at the start"]
    assert free["condition_number"] > 1e4 and free["least_determined"]["name"].startswith("B0_")
    assert free["least_determined"]["std"] > 0.005  # m: B0 not determined to 5 mm by 63 poses
    assert held["condition_number"] < 1e3
    assert held["mean_error_m"] < free["mean_error_m"]


def test_fidelity_rows_of_the_run(solved):
    rows = d1_rows({"d1_error_models": None, "d1_error_models_thesis": extract(solved[2])})
    assert any("Tables 5.2/5.3: D1 error models 1-5" in r[0] and "[d1_error_models_thesis]" in r[0] for r in rows)
    assert sum("Table 5.3: D1 model" in r[0] and "thesis]" in r[0] for r in rows) == 5


def test_the_declared_cyclic_period_generates_the_data():
    p = load_problem(FILE)
    d = p.declaration
    errors = ActuatorErrors.table_4_1(cyclic_period_m=0.0094248)
    again = synthetic_measurements(d.truth, d.measurements.q, noise="laser_tracker", actuator_errors=errors, seed=0)
    assert np.abs(again.T - d.measurements.T).max() < 1e-12
    other = synthetic_measurements(d.truth, d.measurements.q, noise="laser_tracker", actuator_errors=ActuatorErrors.table_4_1(), seed=0)
    assert np.abs(other.T - d.measurements.T).max() > 1e-5


def test_model_5_joins_the_calibrated_arms(solved):
    # Table 5.3 model 5: arms 1, 3 of model 3 and arm 2 of model 4; evaluated on the same validation poses
    models = solved[1]
    m5 = models["5"]
    assert m5["status"] == "optimal" and "arms 1: 3: six-link" in m5["message"]
    assert m5["mean_error_m"] < models["3"]["mean_error_m"]
    assert models["5, arms 1 and 3 with B0 held"]["mean_error_m"] < m5["mean_error_m"]


def test_errors_csv_has_one_header_per_column_with_commas_in_model_names(solved):
    rows = list(csv.reader((solved[3] / "errors.csv").open(encoding="utf-8")))
    assert len(rows[0]) == len(rows[1]) == 1 + len(solved[1])
    assert rows[0][1] == "error_m[1: 3-link, linear actuators]"
