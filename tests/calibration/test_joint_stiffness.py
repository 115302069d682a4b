"""Joint-stiffness calibration, CP vs DPP, on synthetic data of Table 2 stiffnesses at Table 1 poses.

Independent references: the true stiffnesses used to generate the data (round trip),
Cvitanic (2021) Tables 1-2 as transcribed in tests/reference/serial_kr500.toml, and the
thesis' qualitative finding (unscaled CP overestimates stiffness; x10 rotation scaling
changes the CP result). Arm: the ILLUSTRATIVE 6R geometry (assumed DH, the thesis has none).

What the seeded studies below establish (truth = Table 2 DPP values, 10 Table 1 poses x 6
load cases of 1 kN / 200 N m, tracker noise 15 um + 6 um/m, rotation noise 0.015 deg):

* exact data: CP (any rotation weight) and DPP all return the truth: the weighting only
  matters when data and model disagree;
* realistic zero-mean measurement noise alone does NOT reproduce the thesis' gap (CP 1.4x
  DPP on joints 1-3, 6.5x on joint 4): all estimators are median-unbiased; x10 scaling
  changes the CP result at noise level (it amplifies the rotation noise); the inverse-noise
  weight (~0.1 m/rad here) scatters least;
* the spindle/tool in series (231 MN/m) is negligible (< 1 %) and would bias towards
  softer joints, not stiffer;
* a measurement point 0.1 m off the modelled TCP biases CP (and DPP) by 10-30 %, stiffer
  or softer depending on the side of the offset;
* an unmodelled rotation-only compliance (rotation seen by the orientation measurement
  without TCP translation, 0.3 MN m/rad: :func:`table_2_scenario`) makes unscaled CP
  (SI residual) overestimate joints 1-2 (median 1.4x, 1.7x over 30 seeds) and x10 scaling
  lowers them below the truth (0.6x, 0.85x), as from Table 2's CP to its CP x10 column; but
  DPP then overestimates even more (~3x): the thesis' DPP < CP ordering is not reproduced;
* with the CP residual in mm and rad (rotation weight 1e-3 in SI) the same data give
  unbiased CP and x10 changes nothing: the Table 2 pattern needs rotations weighed like
  m against rad;
* the complementary stiffness K_c of eq. (2) at 5 kN / 1 kN m changes the estimates by < 5 %,
  10 % force noise (errors in variables) by ~1 %: neither explains Table 2.
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from gtmodel.calibration.joint_stiffness import (
    ROTATION_WEIGHT_FOR_UNITS,
    TABLE_1_POSES_DEG,
    TABLE_2_K_THETA,
    DeflectionData,
    DeflectionNoise,
    axis_wrenches,
    calibrate_cp,
    calibrate_dpp,
    cp_dpp_study,
    synthetic_deflections,
    table_2_scenario,
)
from gtmodel.errors import InputError
from gtmodel.robots.serial import load_serial_arm

from ..conftest import SHARED_REFERENCE

EXACT_RELATIVE = 1e-8  # round trip on noise-free data
NOISE_MEDIAN_BIAS = 0.10  # |median k / k_true - 1| under noise only
N_SEEDS = 30
WEIGHTING_CHANGE = 0.05  # x10 scaling moves some CP joint 1-3 estimate by more than this
SPINDLE_SHIFT = 0.01  # effect of the 231 MN/m series spindle
OVERESTIMATE = 1.2  # median CP / truth on joints 1-2 in the Table 2 scenario
X10_LOWERING = 0.7  # median CP x10 / median CP on joints 1-2 in the Table 2 scenario
UNIT_WEIGHT_BIAS = 0.05  # |median k / k_true - 1| with the residual in mm and rad
KC_BIAS = 0.05  # complementary stiffness at 5 kN, noise-free
FORCE_NOISE_BIAS = 0.05  # 10 % force noise, median over seeds
STD_FACTOR = 1.6  # reported std vs Monte-Carlo scatter (30 seeds)

K_TRUE = TABLE_2_K_THETA["DPP"]


@pytest.fixture(scope="module")
def arm():
    return load_serial_arm("serial_6r_illustrative")


@pytest.fixture(scope="module")
def loads():
    idx, F = axis_wrenches(10, 1000.0, 200.0)
    return np.radians(TABLE_1_POSES_DEG)[idx], F


#: The three calibrations of Table 2: CP (rotation weight 1 and 10) and DPP.
CALIBRATIONS = {
    "CP": lambda arm, data, **kw: calibrate_cp(arm, data, **kw),
    "CP_x10": lambda arm, data, **kw: calibrate_cp(arm, data, rotation_weight=10.0, **kw),
    "DPP": lambda arm, data, **kw: calibrate_dpp(arm, data, **kw),
}


def test_table_1_matches_reference():
    """Table 1 poses equal the transcribed reference (degrees -> rad at the boundary)."""
    ref = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["static_stiffness"]
    np.testing.assert_array_equal(TABLE_1_POSES_DEG, ref["calibration_poses_deg"]["theta"])


@pytest.mark.parametrize("key", ["CP", "DPP", "CP_rotations_scaled_x10"])
def test_table_2_matches_reference(key):
    """Table 2 stiffnesses equal the transcribed reference (MN m/rad -> N m/rad)."""
    ref = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["static_stiffness"]
    np.testing.assert_allclose(TABLE_2_K_THETA[key], np.array(ref[key]) * 1e6, rtol=1e-15)


@pytest.mark.parametrize("method", list(CALIBRATIONS))
@pytest.mark.parametrize("table", ["CP", "DPP", "CP_rotations_scaled_x10"])
def test_exact_data_round_trip(arm, loads, table, method):
    """Noise-free data: CP (weights 1 and 10) and DPP recover the generating Table 2 values."""
    th, F = loads
    k = TABLE_2_K_THETA[table]
    data = synthetic_deflections(arm, th, F, k, noise=DeflectionNoise(0, 0, 0))
    res = CALIBRATIONS[method](arm, data)
    assert res.success and res.status == "optimal", res.message
    np.testing.assert_allclose(res.k_theta, k, rtol=EXACT_RELATIVE)


@pytest.mark.parametrize("method", ["CP", "DPP"])
def test_positive_bounds_round_trip(arm, loads, method):
    """bounds='positive' (scipy lsq_linear, c >= 0) returns the truth on exact data too."""
    th, F = loads
    data = synthetic_deflections(arm, th, F, K_TRUE, noise=DeflectionNoise(0, 0, 0))
    res = CALIBRATIONS[method](arm, data, bounds="positive")
    assert res.success
    np.testing.assert_allclose(res.k_theta, K_TRUE, rtol=1e-6)


@pytest.fixture(scope="module")
def noise_study(arm, loads):
    th, F = loads
    out = {"cp1": [], "cp10": [], "dpp": [], "cp01": []}
    for seed in range(N_SEEDS):
        d = synthetic_deflections(arm, th, F, K_TRUE, seed=seed)
        out["cp01"].append(calibrate_cp(arm, d, rotation_weight=0.1).k_theta)
        out["cp1"].append(calibrate_cp(arm, d).k_theta)
        out["cp10"].append(calibrate_cp(arm, d, rotation_weight=10.0).k_theta)
        out["dpp"].append(calibrate_dpp(arm, d).k_theta)
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("method", ["cp1", "dpp"])
def test_noise_alone_does_not_bias(noise_study, method):
    """Tracker noise 15 um + 6 um/m, 0.015 deg: median estimates within 10 % of the truth.

    So measurement noise alone does not reproduce the thesis' CP > DPP gap.
    """
    ratio = np.median(noise_study[method], axis=0) / K_TRUE
    assert np.all(np.abs(ratio - 1) < NOISE_MEDIAN_BIAS), ratio


@pytest.mark.parametrize("weight", [1.0, 10.0])
def test_reported_std_matches_monte_carlo(arm, loads, noise_study, weight):
    """The reported std of 1/k (seed 0) agrees with the Monte-Carlo scatter within a factor 1.6."""
    th, F = loads
    d = synthetic_deflections(arm, th, F, K_TRUE, seed=0)
    res = calibrate_cp(arm, d, rotation_weight=weight)
    mc = np.std(1 / noise_study["cp1" if weight == 1.0 else "cp10"], axis=0)
    ratio = res.std_compliance / mc
    assert np.all((ratio > 1 / STD_FACTOR) & (ratio < STD_FACTOR)), ratio


def test_inverse_noise_weighting_beats_x10(noise_study):
    """Weight = translation/rotation noise (~40 um / 0.37 mrad ~ 0.1 m/rad) scatters least on joints 1-3.

    Reference: weighted least squares is most efficient with inverse-noise weights (Gauss-Markov);
    the thesis' x10 goes the other way and is the noisiest here.
    """
    spread = {k: np.std(1 / v, axis=0) * K_TRUE for k, v in noise_study.items()}  # relative std of compliances
    assert np.all(spread["cp01"][:3] < spread["cp1"][:3])
    assert np.all(spread["cp1"][:3] < spread["cp10"][:3])


def test_rotation_scaling_changes_cp_result(arm, loads):
    """x10 rotation weighting moves the CP estimate of joints 1-3 on the same noisy data (seed 0)."""
    th, F = loads
    d = synthetic_deflections(arm, th, F, K_TRUE, seed=0)
    k1 = calibrate_cp(arm, d).k_theta
    k10 = calibrate_cp(arm, d, rotation_weight=10.0).k_theta
    assert np.max(np.abs(k10[:3] / k1[:3] - 1)) > WEIGHTING_CHANGE, (k1, k10)


def test_series_spindle_is_negligible(arm, loads):
    """The 231 MN/m spindle in series changes CP by < 1 % and towards softer joints (same seed)."""
    th, F = loads
    d0 = synthetic_deflections(arm, th, F, K_TRUE, noise=DeflectionNoise(0, 0, 0))
    d1 = synthetic_deflections(arm, th, F, K_TRUE, noise=DeflectionNoise(0, 0, 0), series_translational_stiffness=231e6)
    k0, k1 = calibrate_cp(arm, d0).k_theta, calibrate_cp(arm, d1).k_theta
    assert np.all(np.abs(k1 / k0 - 1) < SPINDLE_SHIFT)
    assert np.all(k1[:3] <= k0[:3] * (1 + 1e-9))


@pytest.fixture(scope="module")
def table_2_study(arm):
    """30 seeds of the Table 2 scenario (rotation-only compliance 0.3 MN m/rad), CP in SI and in mm/rad."""
    mm_rad = ROTATION_WEIGHT_FOR_UNITS["mm_rad"]
    return cp_dpp_study(arm, lambda s: table_2_scenario(arm, s), K_TRUE, seeds=N_SEEDS, rotation_weights=(1.0, 10.0, mm_rad, 10 * mm_rad))


def test_table_2_scenario_reproduces_unscaled_cp_overestimation(table_2_study):
    """Mechanism: unmodelled rotation-only compliance (0.3 MN m/rad), residual in SI (m, rad); 30 seeds.

    Reference: Cvitanic (2021), Table 2: unscaled CP is stiffer than DPP on joints 1-3
    (1.37x, 1.47x, 1.66x) and the x10 rotation scaling lowers joints 1-3 below DPP (0.74x,
    0.67x, 0.67x). Reproduced on joints 1-2: the median unscaled CP overestimates the truth
    by more than OVERESTIMATE and x10 lowers it by more than X10_LOWERING, below the truth.
    Joint 3 is not reproduced (both CP results underestimate it).
    """
    cp1 = np.median(table_2_study["CP w=1"], axis=0)
    cp10 = np.median(table_2_study["CP w=10"], axis=0)
    assert np.all(cp1[:2] > OVERESTIMATE), cp1
    assert np.all(cp10[:2] < X10_LOWERING * cp1[:2]), (cp1, cp10)
    assert np.all(cp10[:2] < 1.0), cp10


def test_table_2_scenario_dpp_is_not_closer_to_truth(table_2_study):
    """Same mechanism and seeds: the thesis' DPP < unscaled CP on joints 1-2 is NOT reproduced.

    DPP's wrist-centre step, eq. (4), transports the extra rotation over the tool lever
    (``dp - dphi x r``) and comes out even stiffer (about 3x the truth). Reference: Table 2
    has DPP below unscaled CP; this test documents the disagreement so that a change of it
    is noticed.
    """
    cp1 = np.median(table_2_study["CP w=1"], axis=0)
    dpp = np.median(table_2_study["DPP"], axis=0)
    assert np.all(dpp[:2] > cp1[:2]), (cp1, dpp)


@pytest.mark.parametrize("scale", [1, 10], ids=["mm_rad", "mm_rad_x10"])
def test_residual_in_mm_and_rad_hides_the_mechanism(table_2_study, scale):
    """Same data, CP residual in mm and rad (rotation weight 1e-3 in SI) and its x10: 30 seeds.

    Reference: with rotations weighing 1000x less the fit is translation-only, and the
    rotation-only compliance is invisible: both CP results are median-unbiased and x10
    changes nothing, unlike Table 2 (x10 changed the result markedly). So the Table 2
    pattern needs a residual in which rotations weigh like m against rad.
    """
    mm_rad = ROTATION_WEIGHT_FOR_UNITS["mm_rad"]
    w = scale * mm_rad
    ratio = np.median(table_2_study[f"CP w={w:g}"], axis=0)
    assert np.all(np.abs(ratio - 1) < UNIT_WEIGHT_BIAS), (w, ratio)


@pytest.mark.parametrize("method", list(CALIBRATIONS))
def test_complementary_stiffness_does_not_explain_table_2(arm, method):
    """Truth with K_c = d(J^T F)/d theta of eq. (2) at 5 kN / 1 kN m loads, noise-free.

    Reference: exact data of the model with K_c kept; the calibrations (eq. (3), K_c
    neglected) deviate by less than KC_BIAS at the Table 1 poses, far from the 40-70 % gap
    of Table 2: the well-conditioned poses make K_c negligible, as the thesis assumed.
    """
    d = table_2_scenario(arm, 0, None, noise=DeflectionNoise(0, 0, 0), force=5000.0, moment=1000.0, complementary=True)
    res = CALIBRATIONS[method](arm, d)
    assert np.all(np.abs(res.k_theta / K_TRUE - 1) < KC_BIAS), res.k_theta / K_TRUE


@pytest.fixture(scope="module")
def force_noise_study(arm):
    noise = DeflectionNoise(force_relative_std=0.10)
    return cp_dpp_study(arm, lambda s: table_2_scenario(arm, s, None, noise=noise), K_TRUE, seeds=N_SEEDS, rotation_weights=(1.0,))


@pytest.mark.parametrize("method", ["CP w=1", "DPP"])
def test_force_noise_dilution_is_small(force_noise_study, method):
    """Errors in variables: 10 % relative force noise on the regressor, 30 seeds.

    Reference: regression dilution biases compliances towards zero by about
    1 / (1 + 0.1^2), i.e. stiffness up by ~1 %: the medians stay within FORCE_NOISE_BIAS,
    far below Table 2's CP/DPP gap.
    """
    assert set(force_noise_study) == {"CP w=1", "DPP"}
    ratios = force_noise_study[method]
    assert np.all(np.abs(np.median(ratios, axis=0) - 1) < FORCE_NOISE_BIAS), np.median(ratios, axis=0)


@pytest.mark.parametrize("side, overestimates", [(+1.0, True), (-1.0, False)], ids=["+x", "-x"])
def test_measurement_point_offset_biases_cp_either_way(arm, loads, side, overestimates):
    """Measured point 0.1 m off the modelled TCP (tool x), tracker noise, seed 0.

    +x: unscaled CP overestimates joints 1-3 by more than 10 % (the thesis' direction);
    -x: it underestimates them. DPP is biased the same way (no CP > DPP ordering).
    """
    from gtmodel.robots.serial import SerialArm

    th, F = loads
    tool = arm.tool.copy()
    tool[:3, 3] += tool[:3, :3] @ np.array([0.1 * side, 0.0, 0.0])
    true_arm = SerialArm(arm.a, arm.alpha, arm.d, arm.theta_offset, tool=tool)
    d = synthetic_deflections(true_arm, th, F, K_TRUE, seed=0)
    ratio = calibrate_cp(arm, d).k_theta[:3] / K_TRUE[:3]
    dpp = calibrate_dpp(arm, d).k_theta[:3] / K_TRUE[:3]
    if overestimates:
        assert np.all(ratio > 1.1) and np.all(dpp > 1.1), (ratio, dpp)
    else:
        assert np.all(ratio < 0.95) and np.all(dpp < 1.0), (ratio, dpp)


def test_result_reports_std_and_residuals(arm, loads):
    """The result carries standard deviations and residual RMS consistent with the noise level."""
    th, F = loads
    d = synthetic_deflections(arm, th, F, K_TRUE, seed=1)
    res = calibrate_cp(arm, d)
    assert res.std_k_theta.shape == (6,) and np.all(np.isfinite(res.std_k_theta))
    assert 1e-6 < res.rms_translation < 1e-4  # tracker noise ~ sqrt(2) * 30 um
    assert res.n_measurements == 60


def test_unexcited_joint_is_reported_not_hidden(arm, loads):
    """Only moments about z at one pose: rank-deficient regressor gives status 'error' with the reason."""
    th, _ = loads
    F = np.tile([0, 0, 0, 0, 0, 100.0], (2, 1))
    d = synthetic_deflections(arm, th[:2], F, K_TRUE, noise=DeflectionNoise(0, 0, 0))
    res = calibrate_cp(arm, d)
    assert not res.success and res.status == "error"
    assert "rank" in res.message


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda a, th, F: DeflectionData(th[:, :5], F, F), r"theta: expected shape \(N, 6\)"),
        (lambda a, th, F: DeflectionData(th, F[:-1], F), "same number of rows"),
        (lambda a, th, F: DeflectionData(th, np.where(np.arange(6) == 2, np.nan, F), F), "F: non-finite value"),
        (lambda a, th, F: DeflectionData(th[:1], F[:1], F[:1]), "at least 2 measurements"),
        (lambda a, th, F: synthetic_deflections(a, th, F, -K_TRUE), "k_theta: expected positive stiffnesses, joint 1"),
        (lambda a, th, F: synthetic_deflections(a, th, F, K_TRUE[:5]), r"k_theta: expected shape \(6\)"),
        (lambda a, th, F: synthetic_deflections(a, th, F, K_TRUE, series_translational_stiffness=0.0), "series_translational_stiffness"),
        (lambda a, th, F: calibrate_cp(a, DeflectionData(th, F, F), rotation_weight=0.0), "rotation_weight"),
        (lambda a, th, F: calibrate_cp(a, DeflectionData(th, F, F), bounds="yes"), "bounds"),
        (lambda a, th, F: calibrate_dpp(a, (th, F, F)), "data: expected a DeflectionData"),
        (lambda a, th, F: DeflectionNoise(position_std=-1.0), "position_std"),
        (lambda a, th, F: axis_wrenches(0), "n_poses"),
    ],
)
def test_bad_input(arm, loads, call, match):
    """Wrong shapes, NaN, non-positive stiffness/weights are refused naming the argument."""
    th, F = loads
    with pytest.raises(InputError, match=match):
        call(arm, th, F)
