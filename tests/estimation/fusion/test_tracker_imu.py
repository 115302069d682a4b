"""Table 7 sensors, sine paths, measurements and the four-point regression (Cvitanic (2021), sec. 4.2).

Independent references: the reference data file (Table 7 as transcribed in
tests/reference/serial_kr500.toml), the design note's R figures (R_p = (6.4 um)^2,
R_a = (0.39e-3)^2 x 1 kHz), finite differences of the closed-form path, the quaternion
kinematics q' = q (x) (0, w) / 2 by finite differences, sample statistics of the noise, and the
regression's closed forms (coefficients [-3, -1, 1, 3] / (10 dt), lag 1.5 dt a, noise
sigma / (sqrt(5) dt)).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import IMU_ROTATION, EndEffectorModel
from gtmodel.estimation.fusion.tracker_imu import (
    SWEEP_PARAMETERS,
    TABLE_7,
    SensorSpec,
    SinePath,
    believed_transform,
    four_point_derivative,
    four_point_velocity,
    mean_error,
    measure,
    orientation_error,
    sensor_only,
)

from ...conftest import SHARED_REFERENCE

REFERENCE = tomllib.loads((SHARED_REFERENCE / "serial_kr500.toml").read_text())["state_estimation"]
DT = 1e-3


def test_table_7_is_the_reference_data():
    # the constants of the package equal the reference file, entry by entry
    assert {k: REFERENCE[k] for k in SWEEP_PARAMETERS} == TABLE_7
    assert SensorSpec.from_reference(REFERENCE) == SensorSpec()


def test_per_sample_noise_matches_the_design_note():
    # design note: R_p = 4.1e-11 m^2 = (6.4 um)^2, R_a = 1.52e-4 = (0.39e-3)^2 * 1 kHz (Appendix B: 4.03e-11, 1.54e-4)
    s = SensorSpec()
    assert s.position_std**2 == pytest.approx(4.096e-11, rel=1e-12)
    assert s.accel_std**2 == pytest.approx(1.521e-4, rel=1e-12)
    assert s.gyro_std == pytest.approx(math.radians(0.0016) * math.sqrt(1000.0), rel=1e-12)
    np.testing.assert_allclose(s.gyro_bias, math.radians(0.0008))


@pytest.mark.parametrize("name", SWEEP_PARAMETERS)
def test_sweep_changes_one_parameter(name):
    specs = SensorSpec().sweep(name)
    assert [getattr(s, name) for s in specs] == [float(v) for v in TABLE_7[name]["offsets"]]
    others = [f for f in SWEEP_PARAMETERS if f != name]
    assert all(getattr(s, f) == getattr(SensorSpec(), f) for s in specs for f in others)


BAD_SPECS = [
    ("negative_noise", {"position_noise_mm": -0.01}, r"position_noise_mm: expected a positive number"),
    ("zero_dt", {"sample_time_s": 0.0}, r"sample_time_s: expected a positive number"),
    ("nan_bias", {"gyro_bias_deg_s": math.nan}, r"gyro_bias_deg_s: expected a finite number"),
    ("text", {"feed_rate_mm_s": "fast"}, r"feed_rate_mm_s: expected a finite number"),
]


@pytest.mark.parametrize("case, kwargs, match", BAD_SPECS, ids=[c[0] for c in BAD_SPECS])
def test_bad_sensor_spec(case, kwargs, match):
    with pytest.raises(InputError, match=match):
        SensorSpec(**kwargs)


BAD_CALLS = [
    ("unknown_sweep", lambda: SensorSpec().sweep("speed"), r"name: expected one of"),
    ("unknown_change", lambda: SensorSpec().replace(speed=1.0), r"changes: expected Table 7 parameters"),
    ("reference_missing", lambda: SensorSpec.from_reference({}), r"table: expected position_noise_mm"),
    ("zero_quaternion", lambda: SinePath(1.0, orientation=(0, 0, 0, 0)), r"orientation: expected a vector of nonzero norm"),
    ("zero_axis", lambda: SinePath(1.0, rotation_axis=(0, 0, 0)), r"rotation_axis: expected a vector of nonzero norm"),
    ("negative_duration", lambda: SinePath(-1.0), r"duration"),
    ("dt_longer_than_path", lambda: SinePath(0.005).truth(0.01), r"dt: expected 10 to 200000 samples over the path's 0.005 s"),
    ("regression_short", lambda: four_point_derivative(np.zeros((3, 2)), DT), r"y: expected shape \(N, d\) with N >= 4"),
    ("error_shapes", lambda: mean_error(np.zeros((3, 2)), np.zeros((3, 3))), r"estimate, truth: expected the same shape"),
    ("measure_wrong_dt", lambda: measure(SinePath(0.1).truth(2e-3), SensorSpec()), r"truth: expected samples spec\.sample_time_s = 0\.001 s apart"),
]


@pytest.mark.parametrize("case, call, match", BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_bad_arguments(case, call, match):
    with pytest.raises(InputError, match=match):
        call()


@pytest.fixture(scope="module")
def measured():
    spec = SensorSpec()
    tr = SinePath(20.0, rotation=True).truth(DT)
    return tr, spec, measure(tr, spec, seed=3)


@pytest.mark.parametrize("part, sl, bias", [("position", slice(0, 3), 0.0), ("gyro", slice(7, 10), "gyro"), ("accelerometer", slice(10, 13), "accel")])
def test_noise_statistics(measured, part, sl, bias):
    # 20001 samples: the mean error is the bias within 4 standard errors, the std the Table 7 figure within 3 %
    tr, spec, m = measured
    clean = np.asarray(EndEffectorModel(DT).measurement.map(tr.t.size)(tr.x.T)).T
    e = m.z[:, sl] - clean[:, sl]
    sigma = {"position": spec.position_std, "gyro": spec.gyro_std, "accelerometer": spec.accel_std}[part]
    b = 0.0 if bias == 0.0 else getattr(spec, f"{bias}_bias")
    np.testing.assert_allclose(e.mean(axis=0), b, atol=4 * sigma / np.sqrt(e.shape[0]))
    np.testing.assert_allclose(e.std(axis=0), sigma, rtol=0.03)


def test_orientation_noise_statistics(measured):
    # the rotation angle of a N(0, s^2 I_3) rotation vector has mean s sqrt(8 / pi) (Maxwell distribution)
    tr, spec, m = measured
    angle = orientation_error(m.quaternion, tr.quaternion)
    assert angle.mean() == pytest.approx(spec.orientation_std * math.sqrt(8 / math.pi), rel=0.03)


def test_four_point_regression_closed_forms():
    # coefficients [-3, -1, 1, 3] / (10 dt); exact on a line; lag 1.5 dt on a parabola
    t = np.arange(20) * DT
    line = np.column_stack([2.0 + 3.0 * t, -t])
    np.testing.assert_allclose(four_point_derivative(line, DT), [[3.0, -1.0]] * 17, rtol=1e-12)
    np.testing.assert_array_equal(four_point_velocity(line, DT), four_point_derivative(line, DT))
    e = np.zeros((4, 1))
    e[3] = 1.0
    assert four_point_derivative(e, DT)[0, 0] == pytest.approx(3 / (10 * DT))
    parabola = (t**2)[:, None]
    np.testing.assert_allclose(four_point_derivative(parabola, DT)[:, 0], 2 * (t[3:] - 1.5 * DT), rtol=1e-9)


def test_four_point_regression_noise():
    # white noise sigma -> slope noise sigma / (sqrt(5) dt)
    rng = np.random.default_rng(0)
    y = rng.normal(0.0, 1e-5, (200_000, 1))
    assert four_point_derivative(y, DT).std() == pytest.approx(1e-5 / (math.sqrt(5) * DT), rel=0.02)


def test_sensor_only_without_noise_is_the_truth_but_for_the_regression():
    # vanishing noise and bias: position, acceleration (lever arm (29) and rotation undone), w exact
    spec = SensorSpec(position_noise_mm=1e-12, orientation_noise_deg=1e-12, gyro_bias_deg_s=0.0, gyro_noise_deg_s_rtHz=1e-12,
                      accel_bias_m_s2=0.0, accel_noise_m_s2_rtHz=1e-12)
    tr = SinePath(1.0, rotation=True).truth(DT)
    se = sensor_only(measure(tr, spec), EndEffectorModel(DT))
    np.testing.assert_allclose(se.position, tr.position[3:], atol=1e-10)
    np.testing.assert_allclose(se.angular_velocity, tr.angular_velocity[3:], atol=1e-10)
    # the regression's lag: 1.5 dt times the derivative (alpha' and the jerk) plus O(dt^2)
    np.testing.assert_allclose(se.angular_acceleration, tr.angular_acceleration[3:], atol=1.5 * DT * 25.1 * 1.01)
    assert np.abs(se.acceleration - tr.acceleration[3:]).max() < 0.01


def test_believed_transform_errors():
    # 2.54 mm along (1, 1, 1)/sqrt(3); a 10 deg turn of R_TI
    t, r = believed_transform(SensorSpec(transform_translation_error_mm=2.54, transform_orientation_error_deg=10.0))
    np.testing.assert_allclose(np.linalg.norm(t - np.array([-0.180, -0.100, 0.120])), 2.54e-3, rtol=1e-12)
    angle = math.degrees(math.acos((np.trace(IMU_ROTATION.T @ r) - 1) / 2))
    assert angle == pytest.approx(10.0, rel=1e-9)


def test_believed_transform_errors_about_a_given_axis():
    # the thesis' axis (its sine's amplitude direction): the translation error along it, the rotation about it
    # (independent: the rotation's fixed axis is the eigenvector of eigenvalue 1 of IMU_ROTATION^T R)
    t, r = believed_transform(SensorSpec(transform_translation_error_mm=2.0, transform_orientation_error_deg=5.0), axis=[0.0, 3.0, 0.0])
    np.testing.assert_allclose(t - np.array([-0.180, -0.100, 0.120]), [0.0, 2e-3, 0.0], atol=1e-15)
    w, v = np.linalg.eig(IMU_ROTATION.T @ r)
    np.testing.assert_allclose(np.abs(np.real(v[:, np.argmin(np.abs(w - 1))])), [0.0, 1.0, 0.0], atol=1e-12)
    with pytest.raises(InputError, match=r"axis: expected a direction of nonzero norm, got \[0\.0, 0\.0, 0\.0\]"):
        believed_transform(SensorSpec(), axis=[0.0, 0.0, 0.0])


def test_mean_error_is_the_mean_norm():
    assert mean_error([[3.0, 4.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]]) == pytest.approx(3.0)
