"""The sine path of Cvitanic (2021), sec. 4.2: closed-form truth (3-axis and 5-axis).

Independent references: finite differences of the closed form, the quaternion kinematics
q' = q (x) (0, w) / 2 by finite differences, the reference sine ``y = A sin(2 pi f x)``.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.estimation.fusion.sine_path import FEED_RATE_M_S, SinePath
from gtmodel.estimation.fusion.tracker_imu import TABLE_7

DT = 1e-3


def test_default_feed_is_the_table_7_baseline():
    assert FEED_RATE_M_S == pytest.approx(TABLE_7["feed_rate_mm_s"]["baseline"] * 1e-3, rel=1e-15)


@pytest.fixture(scope="module")
def five_axis():
    return SinePath(1.5, rotation=True, orientation=(0.9, 0.1, -0.2, 0.3))


@pytest.mark.parametrize("lo, hi, d", [(0, 3, 3), (3, 6, 6)], ids=["p->v", "v->a"])
def test_truth_derivatives_match_finite_differences(five_axis, lo, hi, d):
    # central differences of the closed form at a fine step
    h = 1e-5
    tr = five_axis.truth(h)
    fd = (tr.x[2:, lo:hi] - tr.x[:-2, lo:hi]) / (2 * h)
    np.testing.assert_allclose(fd, tr.x[1:-1, d:d + 3], atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_quaternion_kinematics_match_the_angular_velocity(five_axis):
    # q' = q (x) (0, w) / 2 with w in the body frame, by central differences
    h = 1e-5
    tr = five_axis.truth(h)
    q, w = tr.x[:, 9:13], tr.x[:, 13:16]
    dq = (q[2:] - q[:-2]) / (2 * h)
    qm, wm = q[1:-1], w[1:-1]
    prod = np.column_stack([-(qm[:, 1:] * wm).sum(1), qm[:, :1] * wm + np.cross(qm[:, 1:], wm)])
    np.testing.assert_allclose(dq, prod / 2, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)


def test_alpha_is_the_derivative_of_w(five_axis):
    h = 1e-5
    tr = five_axis.truth(h)
    np.testing.assert_allclose((tr.x[2:, 13:16] - tr.x[:-2, 13:16]) / (2 * h), tr.x[1:-1, 16:19], atol=1e-5)


def test_path_is_the_reference_sine():
    # y = A sin(2 pi f x) along the path, x at the feed rate; 0.833 Hz at 42.33 mm/s
    tr = SinePath(2.0).truth(DT)
    x, y = tr.position[:, 0] - 1.5, tr.position[:, 1]
    np.testing.assert_allclose(y, 0.0762 * np.sin(2 * np.pi * 19.685 * x), atol=1e-15)
    assert SinePath(2.0).omega / (2 * np.pi) == pytest.approx(19.685 * 0.04233)


