"""The fusion study of Cvitanic (2021), sec. 4.2-4.3: one case per motion, the NEES test, the tables' structure.

Independent references: the chi-square distribution (scipy.stats) for the NEES test on
synthetic sequences; the thesis' structure (Table 8 with its own Appendix B Q: fusion passes the
tracker position through unchanged; the velocity improved most, here judged as >= 30 % below the
four-point regression; Table 9: a 10x-noisier tracker is helped but does not reach the baseline
tracker); the errors recomputed from the runs' series (a second reading).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.fusion.runs import nees_test
from gtmodel.estimation.fusion.study import APPENDIX_B, THESIS_TABLE_11, THESIS_TABLE_8, FusionStudy
from gtmodel.estimation.fusion.tracker_imu import SensorSpec
from gtmodel.status import Status

from ...conftest import SHARED_REFERENCE

REFERENCE = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["state_estimation"]
#: The judged velocity improvement over the four-point regression [%].
VELOCITY_IMPROVEMENT = 30.0


def test_thesis_figures_are_the_reference_data():
    # Appendix B, Tables 8 and 11 as transcribed in the reference file (nan: no entry)
    assert list(APPENDIX_B["Q_diag"]) == REFERENCE["Q_diag"] and list(APPENDIX_B["R_diag"]) == REFERENCE["R_diag"]
    ref8 = {k.replace("mean_error_", ""): v for k, v in REFERENCE["table_8"].items()}
    ours8 = {k: {w: [math.nan if x is None else x for x in v[w]] for w in v} for k, v in THESIS_TABLE_8.items()}
    assert set(ours8) == set(ref8)
    np.testing.assert_array_equal([ours8[k][w] for k in ours8 for w in ("sensor", "fusion")], [ref8[k][w] for k in ours8 for w in ("sensor", "fusion")])
    assert {k: {w: list(x) for w, x in v.items()} for k, v in THESIS_TABLE_11.items() if k != "feed_rates_mm_s"} == REFERENCE["table_11"]


@pytest.fixture(scope="module")
def study():
    return FusionStudy(duration=3.0, seed=1)  # the shipped file's baseline


@pytest.fixture(scope="module")
def three_axis(study):
    return study.run_case(False, label="3-axis")


@pytest.fixture(scope="module")
def five_axis(study):
    return study.run_case(True, label="5-axis")


@pytest.mark.parametrize("motion", ["three_axis", "five_axis"])
def test_fused_velocity_beats_the_four_point_regression(request, motion):
    # judged: fused velocity mean error >= 30 % below the tracker-only regression (thesis: up to 95 %)
    e = request.getfixturevalue(motion).errors["velocity_mm_s"]
    assert 100 * (e["sensor"] - e["fusion"]) / e["sensor"] >= VELOCITY_IMPROVEMENT


@pytest.mark.parametrize("motion", ["three_axis", "five_axis"])
def test_errors_are_the_mean_of_the_series(request, motion):
    # a second reading: the per-sample norms of FusionRun.series averaged
    case = request.getfixturevalue(motion)
    assert case.status is Status.COMPLETED and case.end == case.truth.t.size
    again = [(np.mean(case.series(q)[1]), np.mean(case.series(q)[2])) for q in case.errors]
    np.testing.assert_allclose(again, [(e["sensor"], e["fusion"]) for e in case.errors.values()], rtol=1e-12)


@pytest.mark.parametrize("motion", ["three_axis", "five_axis"])
def test_fusion_does_not_degrade_the_measured_position(request, motion):
    # Table 8: fused position not worse than the tracker (by more than 10 %)
    e = request.getfixturevalue(motion).errors["position_mm"]
    assert e["fusion"] <= 1.10 * e["sensor"]


@pytest.mark.xfail(strict=True, reason="not reproduced: Table 8's 'no change' in position (0.0089 mm both). With the white-jerk Q "
                   "the accelerometer smooths the tracker: the fused position error is ~23 % of the tracker's (measured 0.0023 vs "
                   "0.0103 mm). The thesis' own Appendix B Q (Q_p = 2.54e-4 m^2 >> R_p) passes the position through unchanged: "
                   "test_appendix_b_q_reproduces_no_change_in_position.")
def test_fused_position_within_10_percent_of_the_tracker(three_axis):
    e = three_axis.errors["position_mm"]
    assert abs(e["fusion"] / e["sensor"] - 1.0) <= 0.10


def test_appendix_b_q_reproduces_no_change_in_position(study):
    # thesis Table 8: fusion = sensor for the position with the thesis' own Q (Appendix B)
    case = study.run_case(False, q_diag=APPENDIX_B["Q_diag"])
    e = case.errors["position_mm"]
    assert e["fusion"] == pytest.approx(e["sensor"], rel=0.01)


def test_less_accurate_tracker_is_helped_but_does_not_reach_the_good_one(study, three_axis):
    # Table 9 structure: noisy fused < noisy tracker, and > the baseline tracker's error
    noisy = study.run_case(False, study.spec.replace(position_noise_mm=0.064, orientation_noise_deg=0.15))
    e = noisy.errors["position_mm"]
    assert three_axis.errors["position_mm"]["sensor"] < e["fusion"] < e["sensor"]


def test_nees_of_the_5_axis_ekf_is_in_its_band(five_axis):
    # filter consistency (nees_test: time average against chi2 with the effective sample count)
    r = nees_test(five_axis.nees(), five_axis.run.dof)
    assert r["passed"], r


@pytest.mark.xfail(strict=True, reason="not reproduced at the shipped seed: the 3-axis KF is conservative (NEES 7.87 < band "
                   "[8.29, 9.74], dof 9): Q's white jerk (the path's largest |jerk|, 10.9 m/s^3) is put on every axis, while "
                   "x (constant feed) and z have none; seeds 2 and 3 give 7.84 (out) and 8.83 (in).")
def test_nees_of_the_3_axis_kf_is_in_its_band(three_axis):
    r = nees_test(three_axis.nees(), three_axis.run.dof)
    assert r["passed"], r


@pytest.mark.xfail(strict=True, reason="not reproduced: the thesis' angular acceleration is ~45 % better EXCEPT at the sine peaks. "
                   "Our 5-axis rotation (theta_0 sin(omega t) about a fixed body axis) has its |alpha| peaks where the angular "
                   "jerk is zero, so the constant-alpha model is exact there: fusion is best AT the peaks (87 % better) and "
                   "68 % better elsewhere (measured, shipped seed).")
def test_angular_acceleration_fusion_is_worse_at_the_peaks(study, five_axis):
    aa = study._angular_acceleration(five_axis)
    assert aa["peaks"]["improvement_percent"] < aa["off_peaks"]["improvement_percent"]


def test_angular_acceleration_improves(study, five_axis):
    # thesis: about 45 % better (we measure more); at least that much here
    assert study._angular_acceleration(five_axis)["all"]["improvement_percent"] >= 45.0


def test_kf_and_ekf_agree_on_the_linear_model(study, three_axis):
    # the EKF graph on the linear 9-D model is the KF (one implementation): the same errors
    ekf = study.run_case(False, filter_name="ekf")
    np.testing.assert_allclose(ekf.run.x, three_axis.run.x, rtol=0, atol=1e-12)


BAD_STUDIES = [
    ("covariance_zero", {"initial_covariance": (1e-10, 0.0, 1e-2, 1e-6, 1e-4, 1e-2)}, r"initial_covariance: expected a positive definite covariance"),
    ("appendix_negative", {"appendix_b_q": (-1.0,) * 9}, r"appendix_b_q: expected a positive definite diagonal covariance"),
    ("sweep_unknown", {"sweep": {"speed": [1.0]}}, r"sweep: expected Table 7 parameters"),
    ("sweep_negative_noise", {"sweep": {"gyro_noise_deg_s_rtHz": [-1.0]}}, r"gyro_noise_deg_s_rtHz: expected a positive number"),
    ("filter_unknown", {"comparison_filters": ("kf", "lms")}, r"comparison_filters: expected some of kf, ekf, ukf, pf"),
    ("dt_longer_than_path", {"duration": 0.005}, r"dt: expected 10 to 200000 samples"),
    ("seed", {"seed": -1}, r"seed: expected a non-negative integer"),
    ("spec", {"spec": {"position_noise_mm": 1.0}}, r"spec: expected a SensorSpec"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD_STUDIES, ids=[c[0] for c in BAD_STUDIES])
def test_bad_study(case, kwargs, match):
    with pytest.raises(InputError, match=match):
        FusionStudy(**kwargs)


def test_kalman_filter_needs_the_linear_model(study):
    with pytest.raises(InputError, match=r"filter_name: the Kalman filter needs the linear 3-axis model"):
        study.run_case(True, filter_name="kf")


def test_sweep_row_marks_where_fusion_stops_paying(study):
    # a 10 deg error of the believed IMU rotation: the fused position is worse than the tracker's
    case = study.run_case(True, SensorSpec(transform_orientation_error_deg=10.0), duration=1.2)
    row = study._row("transform_orientation_error_deg", 10.0, case)
    assert "position_mm" in row["stops_paying"] and row["position_mm"]["improvement_percent"] < 0
