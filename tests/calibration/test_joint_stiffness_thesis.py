"""The thesis' joint-stiffness set-up (Cvitanic (2021), section 3.2.1, Table 2): loads, three-target rotation noise, DPP's eq. (5), the Table 2 verdicts.

Independent references: the true stiffnesses of noise-free synthetic data (every method must
return them); a Kabsch rigid fit (:meth:`scipy.spatial.transform.Rotation.align_vectors`) of noisy
targets for the rotation noise; hand-made ratio tables for the summary.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel.calibration.joint_stiffness import (
    TABLE_1_POSES_DEG,
    TABLE_2_K_THETA,
    DeflectionNoise,
    calibrate_dpp,
    synthetic_deflections,
)
from gtmodel.calibration.joint_stiffness_thesis import (
    THESIS_RATIO_CP_OVER_DPP,
    gravity_pulley_wrenches,
    summarise_table_2,
    three_target_rotation_std,
)
from gtmodel.errors import InputError
from gtmodel.robots.serial import load_serial_arm

EXACT_RELATIVE = 1e-8
#: Monte-Carlo standard deviation of the Kabsch fit against the closed form (2000 draws: ~3 % scatter).
KABSCH_RTOL = 0.08


@pytest.fixture(scope="module")
def arm():
    return load_serial_arm("serial_6r_illustrative")


def test_gravity_pulley_loads_are_forces_down_and_along_x_and_y():
    idx, F = gravity_pulley_wrenches(10, 500.0)
    assert idx.tolist() == [i for i in range(10) for _ in range(3)]
    assert not F[:, 3:].any()
    np.testing.assert_array_equal(F[:3, :3], [[0, 0, -500.0], [500.0, 0, 0], [0, 500.0, 0]])


@pytest.mark.parametrize("step2", ["rotation", "tcp_translation"])
def test_dpp_recovers_the_truth_from_exact_force_only_data(arm, step2):
    idx, F = gravity_pulley_wrenches(len(TABLE_1_POSES_DEG), 1000.0)
    k = TABLE_2_K_THETA["DPP"]
    data = synthetic_deflections(arm, np.radians(TABLE_1_POSES_DEG)[idx], F, k, noise=DeflectionNoise(0.0, 0.0, 0.0))
    r = calibrate_dpp(arm, data, step2=step2)
    assert r.status == "optimal" and r.extra["step2"] == step2
    np.testing.assert_allclose(r.k_theta, k, rtol=EXACT_RELATIVE)


def test_three_target_rotation_noise_matches_a_kabsch_fit():
    rng = np.random.default_rng(3)
    sigma, radius = 15e-6, 0.15
    ang = np.radians([90.0, 210.0, 330.0])
    targets = radius * np.column_stack([np.cos(ang), np.sin(ang), np.zeros(3)])
    rotvec = np.array([Rotation.align_vectors(targets + sigma * rng.standard_normal((3, 3)), targets)[0].as_rotvec() for _ in range(2000)])
    std = rotvec.std(axis=0)
    assert max(std) == pytest.approx(three_target_rotation_std(sigma, radius), rel=KABSCH_RTOL)
    assert std[2] == pytest.approx(sigma / (radius * math.sqrt(3.0)), rel=KABSCH_RTOL)  # about the normal


def test_summary_of_a_table_2_like_outcome():
    cp = np.tile(THESIS_RATIO_CP_OVER_DPP, (4, 1))
    dpp = np.ones((4, 6))
    scaled = np.full((4, 6), 0.8)
    s = summarise_table_2({"CP": cp, "CPx10": scaled, "DPP": dpp}, "CP", "CPx10")
    assert s["seeds"] == 4 and s["dpp_closer_fraction"] == 1.0
    assert s["dpp_below_cp_every_joint"] and s["cp_scaled_below_dpp_joints_1_3"] and s["dpp_closer_to_truth"]
    np.testing.assert_allclose(s["median_cp_over_dpp"], [3.93 / 2.86, 3.46 / 2.36, 2.77 / 1.67, 1.57 / 0.24, 0.24 / 0.16, 0.17 / 0.14])
    assert s["DPP"]["mean_abs_log_ratio"] == 0.0 and s["CPx10"]["mean_abs_log_ratio"] == pytest.approx(-math.log(0.8))


BAD = [
    ("wrenches_no_pose", lambda arm: gravity_pulley_wrenches(0), r"n_poses: expected an integer >= 1, got 0"),
    ("wrenches_negative_force", lambda arm: gravity_pulley_wrenches(2, -1.0), r"force: expected a finite number > 0, got -1\.0"),
    ("targets_zero_radius", lambda arm: three_target_rotation_std(1e-5, 0.0), r"radius: expected a finite number > 0, got 0\.0"),
    ("targets_negative_noise", lambda arm: three_target_rotation_std(-1e-5, 0.1), r"position_std: expected a finite number >= 0"),
    ("summary_missing_method", lambda arm: summarise_table_2({"CP": np.ones((2, 6))}, "CP", "CPx10"), r"ratios: expected a 'CPx10' entry"),
    ("summary_wrong_shape", lambda arm: summarise_table_2({k: np.ones((2, 5)) for k in ("CP", "X", "DPP")}, "CP", "X"),
     r"ratios\['CP'\]: expected shape \(seeds, 6\), got \(2, 5\)"),
    ("dpp_unknown_step2", lambda arm: calibrate_dpp(arm, synthetic_deflections(arm, np.zeros((2, 6)) + 0.3, np.ones((2, 6)), np.ones(6)), step2="moment"),
     r"step2: expected one of rotation, tcp_translation, got 'moment'"),
]


@pytest.mark.parametrize("case, call, match", BAD, ids=[c[0] for c in BAD])
def test_bad_input(arm, case, call, match):
    with pytest.raises(InputError, match=match):
        call(arm)
