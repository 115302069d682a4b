"""The controllers behind a robot's position interface: Cvitanic's pose correction, the streamed reference with ILC.

References: the laws written out by hand from Cvitanic (2021), sec. 5, eq. (33)
(``u_k = u_{k-1} + K (r_k - p_k)``, saturated) and Dressler (2012), eq. 7.2 (``r_k + c_k``,
``k = floor(t / dt)`` held at the ends), and the closed loop of the correction on the thesis'
delay model solved by python-control (the step's Function inside a 13-cycle delay is stable
exactly where the characteristic polynomial ``z^13 (z - 1) + K`` has its roots inside the unit circle).
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.errors import InputError


def test_pose_correction_adds_the_gain_times_the_error():
    c = PoseCorrection(gain=[0.1, 0.05, 0.0], limit=[5.0, 5.0, 5.0])
    r, p, u_last = np.array([100.0, 200.0, 300.0]), np.array([0.099, 0.2002, 0.31]), np.array([0.5, -0.5, 1.0])
    u, ok = c.function()(0.0, np.r_[r, p], u_last)
    expected = u_last + np.array([0.1, 0.05, 0.0]) * (r - 1000.0 * p)  # hand-written eq. (33)
    np.testing.assert_allclose(np.asarray(u).ravel(), expected, rtol=0, atol=1e-12)
    assert float(ok) == 1.0


def test_pose_correction_takes_the_sent_corrections_out_of_rsol():
    c = PoseCorrection(gain=[0.2, 0.2, 0.2], limit=[5.0, 5.0, 5.0], reference_includes_correction=True)
    u_last = np.array([1.0, 2.0, -1.0])
    r = np.array([10.0, 20.0, 30.0])
    u, _ = c.function()(0.0, np.r_[r + u_last, r / 1000.0], u_last)  # the TCP on the programmed pose: no new correction
    np.testing.assert_allclose(np.asarray(u).ravel(), u_last, atol=1e-12)


@pytest.mark.parametrize("bad, expected_ok", [(np.nan, 0.0), (np.inf, 0.0), (1e5, 1.0)])
def test_pose_correction_saturates_and_flags_non_finite(bad, expected_ok):
    c = PoseCorrection(gain=[1.0, 1.0, 1.0], limit=[2.0, 3.0, 4.0])
    u, ok = c.function()(0.0, [0.0, 0.0, 0.0, bad, 0.0, 0.0], [0.0, 0.0, 0.0])
    assert float(ok) == expected_ok
    assert np.all(np.abs(np.asarray(u).ravel()) <= [2.0, 3.0, 4.0])


@pytest.mark.parametrize("kwargs, match", [
    ({"gain": [0.1, 0.1], "limit": [1, 1, 1]}, "gain: expected a number or shape"),
    ({"gain": [0.1, 1.5, 0.0], "limit": [1, 1, 1]}, r"gain: expected gains in \[0, 1\]"),
    ({"gain": [0.1, -0.1, 0.0], "limit": [1, 1, 1]}, r"gain: expected gains in \[0, 1\]"),
    ({"gain": [0.1, 0.1, 0.1], "limit": [1, 0, 1]}, "limit: expected values > 0"),
    ({"gain": [0.1, 0.1, 0.1], "limit": [1, 1, 1], "dt": 0.0}, "dt: expected"),
    ({"gain": [0.1, 0.1, 0.1], "limit": [1, 1, 1], "dt": 2.0}, r"dt: expected a loop period in \(0, 1\]"),
    ({"gain": [0.1, 0.1, 0.1], "limit": [1, 1, 1], "sensor_scale": -1.0}, "sensor_scale"),
])
def test_pose_correction_refuses(kwargs, match):
    with pytest.raises(InputError, match=match):
        PoseCorrection(**kwargs)


def _closed_loop_stable(gain: float, delay: int = 13, cycles: int = 3000) -> bool:
    """The correction's Function in the loop of eq. (33): a unit step of the path, a pure 13-cycle delay to the TCP."""
    c = PoseCorrection(gain=[gain, 0.0, 0.0], limit=[1e3, 1e3, 1e3])
    f = c.function()
    u = np.zeros(3)
    sent = [0.0] * delay
    errors = []
    for _ in range(cycles):
        p = sent[-delay]  # the TCP follows the correction 13 cycles later
        u = np.asarray(f(0.0, [1.0, 0.0, 0.0, p / 1000.0, 0.0, 0.0], u)[0]).ravel()
        sent.append(float(u[0]))
        errors.append(1.0 - p)
    return bool(abs(errors[-1]) < 1e-3)


@pytest.mark.parametrize("gain", [0.05, 0.1, 0.15])
def test_pose_correction_in_the_delayed_loop_is_stable_where_the_poles_say(gain):
    # python-control: the loop K z/(z-1) z^-13 closed, its poles = roots of z^13 (z - 1) + K
    loop = control.feedback(control.tf([gain, 0], [1, -1], dt=True) * control.tf([1], [1] + [0] * 13, dt=True), 1)
    stable_by_poles = bool(np.max(np.abs(control.poles(loop))) < 1.0)
    assert _closed_loop_stable(gain) == stable_by_poles


def test_streaming_reads_row_k_and_holds_the_ends():
    ref = np.cumsum(np.ones((10, 2)), axis=0)
    corr = 0.1 * np.ones((10, 2))
    s = ReferenceStreaming(ref, corr, dt=0.004)
    f = s.function()
    rows = {0.0: 0, 0.0041: 1, 0.0399: 9, 5.0: 9, -1.0: 0}
    got = {t: np.asarray(f(t, [0.0, 0.0], [0.0, 0.0])[0]).ravel() for t in rows}
    np.testing.assert_allclose(np.array(list(got.values())), np.array([ref[k] + 0.1 for k in rows.values()]), atol=1e-12)


def test_streaming_saturates_at_its_bounds():
    ref = np.zeros((5, 1))
    s = ReferenceStreaming(ref, np.full((5, 1), 50.0), lower=[-1.0], upper=[2.0])
    assert float(s.function()(0.0, [0.0], [0.0])[0]) == 2.0
    assert float(s.function()(np.nan, [0.0], [0.0])[1]) == 0.0


@pytest.mark.parametrize("kwargs, match", [
    ({"reference": np.zeros((4, 2)), "correction": np.zeros((3, 2))}, "correction: expected the reference's shape"),
    ({"reference": np.array([[0.0, np.nan]])}, "reference"),
    ({"reference": np.zeros((4, 2)), "lower": [1.0, 1.0], "upper": [0.0, 0.0]}, "lower, upper: expected lower <= upper"),
    ({"reference": np.full((4, 1), 5.0), "lower": [0.0], "upper": [1.0]}, "reference: expected every row within the bounds"),
    ({"reference": np.zeros((4, 2)), "names": ["a"]}, "names, feedback_names: expected 2 names"),
])
def test_streaming_refuses(kwargs, match):
    with pytest.raises(InputError, match=match):
        ReferenceStreaming(**kwargs)
